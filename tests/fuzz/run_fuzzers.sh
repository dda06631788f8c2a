#!/usr/bin/env bash
# Builds and runs the libFuzzer harnesses of tests/fuzz (clang, ASan + UBSan).
#   tests/fuzz/run_fuzzers.sh build FUZZ_BUILD_DIR            configure + build (clang++-14 or clang++)
#   tests/fuzz/run_fuzzers.sh run FUZZ_BUILD_DIR NAME SECONDS run fuzz_NAME (csv, pipeline, device)
# ctest runs `build` once and each harness for DRIFTLAB_FUZZ_SECONDS (default 60). A longer run
# for developers (an hour each, new inputs kept in the build directory):
#   tests/fuzz/run_fuzzers.sh build build-fuzz && tests/fuzz/run_fuzzers.sh run build-fuzz csv 3600
# A finding (crash, sanitizer report, violated property, uncaught exception) fails the run and
# leaves the input in FUZZ_BUILD_DIR/findings/<name>/; reproduce with build-fuzz/tests/fuzz/fuzz_NAME FILE.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
source_dir=$(cd "$here/../.." && pwd)
mode=${1:?usage: run_fuzzers.sh build|run FUZZ_BUILD_DIR [NAME SECONDS]}
build_dir=${2:?fuzz build directory}

case "$mode" in
build)
  cxx=$(command -v clang++-14 || command -v clang++ || true)
  [[ -n "$cxx" ]] || { echo "run_fuzzers.sh: clang++ not found (apt-get install clang)" >&2; exit 1; }
  launcher=()
  command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  # Build type "Fuzz" (no preset flags): -O1 and line tables only, the quickest build that still
  # fuzzes fast and gives symbolized stack traces. MRPT is left out (no harness needs it).
  cmake -S "$source_dir" -B "$build_dir" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=Fuzz \
    -DDRIFTLAB_BUILD_TESTS=OFF -DDRIFTLAB_BUILD_BENCH=OFF -DDRIFTLAB_BUILD_FUZZERS=ON -DDRIFTLAB_WITH_MRPT=OFF \
    "${launcher[@]}" \
    -DCMAKE_CXX_FLAGS="-O1 -gline-tables-only -fsanitize=address,undefined,fuzzer-no-link -fno-sanitize-recover=undefined -fno-omit-frame-pointer" \
    >/dev/null
  cmake --build "$build_dir" -j "${JOBS:-2}" --target fuzzers
  ;;
run)
  name=${3:?harness name: csv, pipeline or device}
  seconds=${4:-60}
  exe="$build_dir/tests/fuzz/fuzz_$name"
  [[ -x "$exe" ]] || { echo "run_fuzzers.sh: $exe not built (run: run_fuzzers.sh build $build_dir)" >&2; exit 1; }
  work="$build_dir/corpus/$name"
  findings="$build_dir/findings/$name"
  mkdir -p "$work" "$findings"
  export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0:abort_on_error=1}
  export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
  # New inputs go to $work (outside the source tree); the seed corpus is read only.
  "$exe" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=2048 -max_len=8192 -print_final_stats=1 \
    -artifact_prefix="$findings/" "$work" "$here/corpus/$name" 2>&1 | tail -n 25
  exit "${PIPESTATUS[0]}"
  ;;
*)
  echo "usage: run_fuzzers.sh build|run FUZZ_BUILD_DIR [NAME SECONDS]" >&2
  exit 2
  ;;
esac
