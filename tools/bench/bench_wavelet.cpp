// Wavelet-threshold denoising benchmark on the standard records' rate channel (rad/s at 100 Hz),
// one core, kernel time only.
//   BM_WaveletDenoise/N   db4 (GSL daubechies k = 8), 5 levels, hybrid SURE, soft, noise from the
//                         finest level; padding to the next power of two, forward + inverse DWT.
#include <benchmark/benchmark.h>

#include "plugins/wavelet/wavelet.hpp"
#include "tools/bench/bench_signals.hpp"

namespace driftlab {
namespace {

void BM_WaveletDenoise(benchmark::State& state) {
  const auto* signal = bench::signal_or_skip(state);
  if (signal == nullptr) return;
  const wavelet::Config config{.rule = wavelet::ThresholdRule::SureHybrid};
  for (auto _ : state) {
    wavelet::Result r = wavelet::denoise(signal->rate_rad_s, config);
    benchmark::DoNotOptimize(r.denoised.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

BENCHMARK(BM_WaveletDenoise)->Arg(100000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace driftlab
