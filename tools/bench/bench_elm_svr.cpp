// ELM and SVR benchmarks on the standard records (bench::regression_problem: temperature and its
// rate as features, the rate as target; feature preparation is not timed). One thread.
//   BM_ElmFit/N          one ridge fit with the defaults (50 sigmoid units).
//   BM_ElmNsga2Fit/N     tune = true with optimizer/pagmo nsga2 at population 16, generations 10
//                        (176 fits on the 80 % training part of at most 20 000 rows, two
//                        objectives: held-out RMSE and ||beta||), then the final fit.
//   BM_SvrFit/N          one dlib SMO fit on the evenly spaced 2000-row subsample (C 10, epsilon
//                        0.1 SD, gamma 0.5) plus predicting one row.
#include <benchmark/benchmark.h>

#include "tools/bench/bench_signals.hpp"

namespace driftlab {
namespace {

void BM_ElmFit(benchmark::State& state) { bench::run_regressor(state, "regressor/elm", {}); }

void BM_ElmNsga2Fit(benchmark::State& state) {
  bench::run_regressor(
      state, "regressor/elm",
      {"tune=true",
       "optimizer={plugin: optimizer/pagmo, params: {algorithm: nsga2, population: 16, generations: 10}}"});
}

void BM_SvrFit(benchmark::State& state) { bench::run_regressor(state, "regressor/svr", {}); }

BENCHMARK(BM_ElmFit)->Arg(10000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ElmNsga2Fit)->Arg(100000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SvrFit)->Arg(10000)->Arg(1000000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace driftlab
