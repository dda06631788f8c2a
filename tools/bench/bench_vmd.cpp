// VMD benchmark on the standard records' rate channel (rad/s at 100 Hz), one core, kernel time only.
//   BM_Vmd/N   K = 5 modes, alpha = 2000, tau = 0, uniform initial centres, tolerance 1e-7, at most
//              500 iterations (the defaults of decomposition/vmd); mirror extension to 2N, FFTW r2c/c2r.
// Counters: iterations (ADMM iterations run; 500 = the cap).
#include <benchmark/benchmark.h>

#include "plugins/vmd/vmd.hpp"
#include "tools/bench/bench_signals.hpp"

namespace driftlab {
namespace {

void BM_Vmd(benchmark::State& state) {
  const auto* signal = bench::signal_or_skip(state);
  if (signal == nullptr) return;
  const vmd::Config config{.modes = 5};
  vmd::Result r;
  for (auto _ : state) {
    r = vmd::decompose(signal->rate_rad_s, config);
    benchmark::DoNotOptimize(r.residue.data());
  }
  state.counters["iterations"] = r.iterations;
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

BENCHMARK(BM_Vmd)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace driftlab
