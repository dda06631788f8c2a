// driftlab-bench: every benchmark of the project (Google Benchmark), named BM_<Kernel>/<N>.
#include <benchmark/benchmark.h>

#include <cstdio>

#include "tools/bench/bench_signals.hpp"

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  if (driftlab::bench::bench_signal_dir().empty()) {
    std::fprintf(stderr,
                 "driftlab-bench: DRIFTLAB_BENCH_SIGNALS is not set. Generate the benchmark signals with\n"
                 "  python3 tools/bench/gen_signals.py --out DIR\n"
                 "and run DRIFTLAB_BENCH_SIGNALS=DIR driftlab-bench\n");
    return 2;
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
