// EMD-family benchmarks on the standard records' rate channel (rad/s at 100 Hz), one core, kernel
// time only (records are loaded before the timed loop).
//   BM_Emd/N      N = 1e3 ... 1e6  EMD with libeemd's default stopping rule: S-number 4, at most
//                                  50 sifts per IMF; mirrored ends; IMFs until the residue has
//                                  fewer than 3 extrema (at most floor(log2 N))
//   BM_Ceemdan/N  N = 1e4          CEEMDAN (Torres 2011), 100 members, eps0 = 0.2, same sifting
// Counters: imfs, sifts (total over the IMFs; CEEMDAN: over the members, noise modes excluded).
#include <benchmark/benchmark.h>

#include <numeric>

#include "plugins/emd/emd.hpp"
#include "tools/bench/bench_signals.hpp"

namespace driftlab {
namespace {

void report(benchmark::State& state, const emd::Result& r) {
  state.counters["imfs"] = static_cast<double>(r.imfs.cols());
  state.counters["sifts"] = static_cast<double>(std::accumulate(r.sifts.begin(), r.sifts.end(), 0L));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_Emd(benchmark::State& state) {
  const auto* signal = bench::signal_or_skip(state);
  if (signal == nullptr) return;
  const emd::EmdConfig config;  // S-number 4, max 50 sifts, mirror ends
  emd::Result r;
  for (auto _ : state) {
    r = emd::emd(signal->rate_rad_s, config);
    benchmark::DoNotOptimize(r.residue.data());
  }
  report(state, r);
}

void BM_Ceemdan(benchmark::State& state) {
  const auto* signal = bench::signal_or_skip(state);
  if (signal == nullptr) return;
  emd::CeemdanConfig config;
  config.ensemble.ensemble_size = 100;
  config.ensemble.noise_strength = 0.2;
  config.ensemble.threads = 1;
  emd::Result r;
  for (auto _ : state) {
    r = emd::ceemdan(signal->rate_rad_s, config);
    benchmark::DoNotOptimize(r.residue.data());
  }
  report(state, r);
}

BENCHMARK(BM_Emd)->Arg(1000)->Arg(10000)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Ceemdan)->Arg(10000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace driftlab
