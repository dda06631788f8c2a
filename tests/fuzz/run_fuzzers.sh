#!/usr/bin/env bash
# Builds and runs the libFuzzer harnesses of tests/fuzz (clang, ASan + UBSan).
#   tests/fuzz/run_fuzzers.sh build FUZZ_BUILD_DIR            configure + build (clang++-14 or clang++)
#   tests/fuzz/run_fuzzers.sh run FUZZ_BUILD_DIR NAME SECONDS   a random campaign of fuzz_NAME
#                                                                (csv, stream, pipeline, device, calibration,
#                                                                ulog, dataflash, mcap, ros_messages; with
#                                                                MRPT also nav_scenario and rawlog)
#   tests/fuzz/run_fuzzers.sh check FUZZ_BUILD_DIR NAME RUNS     a reproducible run: seed 1, RUNS
#                                                                inputs, from the seed corpus only
# ctest runs `build` once and `check` for each harness with DRIFTLAB_FUZZ_RUNS inputs: the same
# inputs on every machine, so the test command passes or fails the same way everywhere (a random
# campaign in CI would fail at random on whatever it happens to find). Random campaigns are for
# developers, before a commit that touches a reader (an hour each, new inputs kept in the build
# directory):
#   tests/fuzz/run_fuzzers.sh build build-fuzz && tests/fuzz/run_fuzzers.sh run build-fuzz csv 3600
# A finding (crash, sanitizer report, violated property, uncaught exception) fails the run and
# leaves the input in FUZZ_BUILD_DIR/findings/<name>/; reproduce with build-fuzz/tests/fuzz/fuzz_NAME FILE.
# A `check` also fails when an input was left there without the run failing (a finding in a child
# process the harness forked, e.g. the rawlog reader's guard).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source_dir=$(cd "$here/../.." && pwd)
mode=${1:?usage: run_fuzzers.sh build|run|check FUZZ_BUILD_DIR [NAME SECONDS|RUNS]}
build_dir=${2:?fuzz build directory}

case "$mode" in
build)
  cxx=$(command -v clang++-14 || command -v clang++ || true)
  [[ -n "$cxx" ]] || { echo "run_fuzzers.sh: clang++ not found (apt-get install clang)" >&2; exit 1; }
  launcher=()
  command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  # Build type "Fuzz" (no preset flags): -O1 and line tables only, the quickest build that still
  # fuzzes fast and gives symbolized stack traces. MRPT as in the main build (AUTO): the nav
  # scenario harness links the MRPT bridge (MRPT's own libraries run uninstrumented).
  cmake -S "$source_dir" -B "$build_dir" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=Fuzz \
    -DDRIFTLAB_BUILD_TESTS=OFF -DDRIFTLAB_BUILD_BENCH=OFF -DDRIFTLAB_BUILD_FUZZERS=ON -DDRIFTLAB_WITH_MRPT=AUTO \
    "${launcher[@]}" \
    -DCMAKE_CXX_FLAGS="-O1 -gline-tables-only -fsanitize=address,undefined,fuzzer-no-link -fno-sanitize-recover=undefined -fno-omit-frame-pointer" \
    >/dev/null
  cmake --build "$build_dir" -j "${JOBS:-2}" --target fuzzers
  ;;
run|check)
  name=${3:?harness name: csv, stream, pipeline, device, calibration, ulog, dataflash, mcap, ros_messages, nav_scenario or rawlog}
  budget=${4:-60}
  exe="$build_dir/tests/fuzz/fuzz_$name"
  [[ -x "$exe" ]] || { echo "run_fuzzers.sh: $exe not built (run: run_fuzzers.sh build $build_dir)" >&2; exit 1; }
  findings="$build_dir/findings/$name"
  if [[ "$mode" == run ]]; then
    work="$build_dir/corpus/$name"
    limits=(-max_total_time="$budget")
  else
    work="$build_dir/check-corpus/$name"
    rm -rf "$work"
    limits=(-seed=1 -runs="$budget" -reload=0)
  fi
  mkdir -p "$work" "$findings"
  export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0:abort_on_error=1}
  export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
  if [[ "$name" == rawlog ]]; then
    # The reader's child process bounds its own memory (fuzz_rawlog.cpp): libFuzzer's per-allocation
    # limit, which would report it as a finding, must not fire there first.
    limits+=(-malloc_limit_mb=1000000000)
  fi
  found_before=$(find "$findings" -type f | wc -l)
  # New inputs go to $work (outside the source tree); the seed corpus is read only.
  "$exe" "${limits[@]}" -timeout=20 -rss_limit_mb=2048 -max_len=8192 -print_final_stats=1 \
    -artifact_prefix="$findings/" "$work" "$here/corpus/$name" 2>&1 | tail -n 25
  status=${PIPESTATUS[0]}
  if [[ "$mode" == check && "$status" == 0 && $(find "$findings" -type f | wc -l) != "$found_before" ]]; then
    echo "run_fuzzers.sh: the run passed but left new inputs in $findings (a finding in a child process)" >&2
    status=1
  fi
  exit "$status"
  ;;
*)
  echo "usage: run_fuzzers.sh build|run|check FUZZ_BUILD_DIR [NAME SECONDS|RUNS]" >&2
  exit 2
  ;;
esac
