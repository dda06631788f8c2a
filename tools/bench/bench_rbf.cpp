// RBF network benchmarks on the standard records.
//   Features: temperature (degC) and its time derivative (degC/s, central difference over
//   +-0.5 s, one-sided at the ends); target: rate (rad/s). Feature preparation is not timed.
//   BM_RbfFit/N     one least-squares fit with the defaults (k-means, K = 20, sigma = 1).
//   BM_RbfGaFit/N   tune = true with optimizer/ga at population 16, generations 10 (156 fits on
//                   the 80 % training part, default search ranges sigma [0.05, 3], centres
//                   [4, 60], log10 regularization [-10, -2]), then the final fit; one thread.
#include <benchmark/benchmark.h>

#include <algorithm>

#include "framework/params_io.hpp"
#include "framework/registry.hpp"
#include "tools/bench/bench_signals.hpp"

namespace driftlab {
namespace {

struct RbfProblem {
  Eigen::MatrixXd features;
  Eigen::VectorXd target;
};

RbfProblem rbf_problem(std::size_t n) {
  const auto& signal = bench::bench_signal(n);
  const Eigen::Index size = signal.temp_c.size();
  const auto half_window = static_cast<Eigen::Index>(std::max(1.0, 0.5 * signal.sample_rate_hz));
  RbfProblem p{Eigen::MatrixXd(size, 2), signal.rate_rad_s};
  p.features.col(0) = signal.temp_c;
  for (Eigen::Index i = 0; i < size; ++i) {
    const Eigen::Index lo = std::max<Eigen::Index>(0, i - half_window);
    const Eigen::Index hi = std::min(size - 1, i + half_window);
    p.features(i, 1) = (signal.temp_c[hi] - signal.temp_c[lo]) / (signal.time_s[hi] - signal.time_s[lo]);
  }
  return p;
}

void run_rbf(benchmark::State& state, const std::vector<std::string>& assignments) {
  RbfProblem problem;
  try {
    problem = rbf_problem(static_cast<std::size_t>(state.range(0)));
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  Registry registry;
  register_builtin_plugins(registry);
  const auto params = params_from_assignments(registry, "regressor/rbf", assignments);
  for (auto _ : state) {
    auto rbf = registry.create_as<Regressor>({"regressor/rbf", params});
    RunContext ctx;
    ctx.threads = 1;
    rbf->fit(problem.features, problem.target, ctx);
    benchmark::DoNotOptimize(rbf->predict(problem.features.topRows(1)));
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_RbfFit(benchmark::State& state) { run_rbf(state, {}); }

void BM_RbfGaFit(benchmark::State& state) {
  run_rbf(state, {"tune=true", "optimizer={plugin: optimizer/ga, params: {population: 16, generations: 10}}"});
}

BENCHMARK(BM_RbfFit)->Arg(10000)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RbfGaFit)->Arg(10000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace driftlab
