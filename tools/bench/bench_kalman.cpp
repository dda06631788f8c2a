// Kalman filter benchmarks on the standard records (rate in rad/s), one core. Noise from the
// generator's Allan terms: R = N^2 fs with N = 0.3 deg/sqrt(h); Q = K^2 / fs with K = 1 deg/h/sqrt(h).
//   BM_Kalman/N               scalar random-walk filter (the paper's model), states only
//   BM_KalmanSmoother/N       the same filter followed by the RTS smoother (stores P per sample)
//   BM_KalmanGaussMarkov/N    random walk + Gauss-Markov (2 states) through the matrix path
#include <benchmark/benchmark.h>

#include "plugins/kalman/kalman.hpp"
#include "framework/units.hpp"
#include "tools/bench/bench_signals.hpp"

namespace driftlab {
namespace {

constexpr double kArw = 0.3 * kRadPerDeg / kSqrtSecondsPerHour;                    // rad/s/sqrt(Hz)
constexpr double kRrw = 1.0 * kRadPerDeg / kSecondsPerHour / kSqrtSecondsPerHour;  // rad/s^2/sqrt(Hz)

const Eigen::VectorXd* rate_or_skip(benchmark::State& state) {
  try {
    return &bench::bench_signal(static_cast<std::size_t>(state.range(0))).rate_rad_s;
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return nullptr;
  }
}

kalman::ScalarModel bench_model(double fs) {
  return {kalman::process_variance_from_rrw(kRrw, fs), kalman::measurement_variance_from_arw(kArw, fs)};
}

void BM_Kalman(benchmark::State& state) {
  const auto* z = rate_or_skip(state);
  if (!z) return;
  const auto model = bench_model(100.0);
  for (auto _ : state) {
    Eigen::VectorXd x = kalman::filter_states(*z, model, (*z)[0], model.r);
    benchmark::DoNotOptimize(x.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_KalmanSmoother(benchmark::State& state) {
  const auto* z = rate_or_skip(state);
  if (!z) return;
  const auto model = bench_model(100.0);
  for (auto _ : state) {
    auto estimates = kalman::smooth(*z, model, (*z)[0], model.r);
    benchmark::DoNotOptimize(estimates.state.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_KalmanGaussMarkov(benchmark::State& state) {
  const auto* rate = rate_or_skip(state);
  if (!rate) return;
  const Eigen::MatrixXd z = *rate;
  const double fs = 100.0;
  const auto scalar = bench_model(fs);
  const auto model = kalman::random_walk_gauss_markov_model(scalar.q, 1e-4, 100.0, 1.0 / fs, scalar.r);
  const Eigen::VectorXd x0 = Eigen::VectorXd::Zero(2);
  const Eigen::MatrixXd p0 = Eigen::MatrixXd::Identity(2, 2);
  for (auto _ : state) {
    auto estimates = kalman::filter(z, model, x0, p0);
    benchmark::DoNotOptimize(estimates.state.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

BENCHMARK(BM_Kalman)->Arg(10000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KalmanSmoother)->Arg(1000000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KalmanGaussMarkov)->Arg(1000000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace driftlab
