// RBF network benchmarks on the standard records (bench::regression_problem: temperature and its
// rate as features, the rate as target; feature preparation is not timed).
//   BM_RbfFit/N     one least-squares fit with the defaults (k-means, K = 20, sigma = 1).
//   BM_RbfGaFit/N   tune = true with optimizer/ga at population 16, generations 10 (156 fits on
//                   the 80 % training part, default search ranges sigma [0.05, 3], centres
//                   [4, 60], log10 regularization [-10, -2]), then the final fit; one thread.
#include <benchmark/benchmark.h>

#include "tools/bench/bench_signals.hpp"

namespace driftlab {
namespace {

void BM_RbfFit(benchmark::State& state) { bench::run_regressor(state, "regressor/rbf", {}); }

void BM_RbfGaFit(benchmark::State& state) {
  bench::run_regressor(state, "regressor/rbf",
                       {"tune=true", "optimizer={plugin: optimizer/ga, params: {population: 16, generations: 10}}"});
}

BENCHMARK(BM_RbfFit)->Arg(10000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RbfGaFit)->Arg(10000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace driftlab
