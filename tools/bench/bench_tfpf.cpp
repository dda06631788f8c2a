// TFPF benchmark on the standard records' rate channel (rad/s at 100 Hz), one core, kernel time only.
//   BM_Tfpf/N   fixed window of 31 samples (rectangular lag window; FFT size 64 for the coarse peak
//               search, then Newton steps), and with the window rule's long window of 65 (FFT 256).
#include <benchmark/benchmark.h>

#include "plugins/tfpf/tfpf.hpp"
#include "tools/bench/bench_signals.hpp"

namespace driftlab {
namespace {

void run(benchmark::State& state, int window) {
  const auto* signal = bench::signal_or_skip(state);
  if (signal == nullptr) return;
  const tfpf::Config config{.rule = tfpf::WindowRule::Fixed, .window = window};
  for (auto _ : state) {
    tfpf::Result r = tfpf::filter(signal->rate_rad_s, config);
    benchmark::DoNotOptimize(r.filtered.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_Tfpf(benchmark::State& state) { run(state, 31); }
void BM_TfpfLongWindow(benchmark::State& state) { run(state, 65); }

BENCHMARK(BM_Tfpf)->Arg(100000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TfpfLongWindow)->Arg(100000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace driftlab
