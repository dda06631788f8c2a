// The benchmark records written by tools/bench/gen_signals.py (static gyro at 100 Hz, one
// thermal cycle per record), read from $DRIFTLAB_BENCH_SIGNALS:
//   gyro_N{1000,10000,100000,1000000}.csv  (t_s, rate_dps, temp_c)
//   gyro_N10000000.f64                     (raw little-endian float64 rate_dps only)
// Loaded once per process and cached; file parsing is never inside a timed region.
#pragma once

#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

namespace driftlab::bench {

struct BenchSignal {
  Eigen::VectorXd time_s;
  Eigen::VectorXd rate_rad_s;
  Eigen::VectorXd temp_c;  // empty for the 1e7 binary record
  double sample_rate_hz = 100.0;
};

// Throws std::runtime_error naming the missing file and how to generate it.
const BenchSignal& bench_signal(std::size_t n);

// The signal of length state.range(0), or nullptr after marking the benchmark skipped with the
// reason (e.g. the signal files are missing).
const BenchSignal* signal_or_skip(benchmark::State& state);

// The directory in $DRIFTLAB_BENCH_SIGNALS, or empty.
std::string bench_signal_dir();

// The regressors' benchmark problem on the record of length n. Features: temperature (degC) and
// its time derivative (degC/s, central difference over +-0.5 s, one-sided at the ends); target:
// rate (rad/s). Throws like bench_signal().
struct RegressionProblem {
  Eigen::MatrixXd features;
  Eigen::VectorXd target;
};
RegressionProblem regression_problem(std::size_t n);

// Times fit (+ one predict) of `plugin` configured by `assignments` (key=value, as on the command
// line) on regression_problem(state.range(0)), one thread; skipped when the signals are missing.
void run_regressor(benchmark::State& state, const std::string& plugin, const std::vector<std::string>& assignments);

}  // namespace driftlab::bench
