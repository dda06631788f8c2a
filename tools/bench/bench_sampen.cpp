// Sample entropy benchmark on the standard records: exact SampEn(m = 2, r = 0.2 x population SD)
// of the rate channel, one core. Timed: the SD, the sorting and the counting.
//   BM_SampEn/N   N = 1e3, 1e4, 1e5
#include <benchmark/benchmark.h>

#include <span>

#include "plugins/sample_entropy/sample_entropy.hpp"
#include "tools/bench/bench_signals.hpp"

namespace driftlab {
namespace {

void BM_SampEn(benchmark::State& state) {
  const Eigen::VectorXd* rate = nullptr;
  try {
    rate = &bench::bench_signal(static_cast<std::size_t>(state.range(0))).rate_rad_s;
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  const std::span<const double> x(rate->data(), static_cast<std::size_t>(rate->size()));
  sampen::Result result;
  for (auto _ : state) {
    result = sampen::sample_entropy_relative(x, 2, 0.2);
    benchmark::DoNotOptimize(result);
  }
  state.counters["sampen"] = result.value;
  state.counters["B_pairs"] = static_cast<double>(result.b);
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

BENCHMARK(BM_SampEn)->Arg(1000)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace driftlab
