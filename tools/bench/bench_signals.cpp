#include "tools/bench/bench_signals.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>

#include "plugins/builtins.hpp"
#include "framework/csv.hpp"
#include "framework/params_io.hpp"
#include "framework/registry.hpp"

namespace driftlab::bench {
namespace {

BenchSignal load(std::size_t n) {
  const auto dir = std::filesystem::path(bench_signal_dir());
  const auto csv = dir / ("gyro_N" + std::to_string(n) + ".csv");
  const auto f64 = dir / ("gyro_N" + std::to_string(n) + ".f64");
  BenchSignal s;
  if (std::filesystem::exists(csv)) {
    CsvReadOptions options;
    options.required_roles = {"rate", "temperature"};
    const auto record = read_csv(csv, options);
    s.time_s = record.time();
    s.rate_rad_s = record.channel("rate").values;
    s.temp_c = record.channel("temperature").values;
    return s;
  }
  if (std::filesystem::exists(f64)) {
    const auto bytes = std::filesystem::file_size(f64);
    s.rate_rad_s.resize(static_cast<Eigen::Index>(bytes / sizeof(double)));
    std::FILE* f = std::fopen(f64.c_str(), "rb");
    const auto got =
        f ? std::fread(s.rate_rad_s.data(), sizeof(double), static_cast<std::size_t>(s.rate_rad_s.size()), f) : 0;
    if (f) std::fclose(f);
    if (got != static_cast<std::size_t>(s.rate_rad_s.size())) throw std::runtime_error("cannot read " + f64.string());
    s.rate_rad_s *= 3.14159265358979323846 / 180.0;
    s.time_s =
        Eigen::VectorXd::LinSpaced(s.rate_rad_s.size(), 0.0, static_cast<double>(s.rate_rad_s.size() - 1) / 100.0);
    return s;
  }
  throw std::runtime_error("benchmark signal " + csv.string() +
                           " (or .f64) not found; generate the signals with\n"
                           "  python3 tools/bench/gen_signals.py --out DIR\nand set DRIFTLAB_BENCH_SIGNALS=DIR");
}

}  // namespace

const BenchSignal* signal_or_skip(benchmark::State& state) {
  try {
    return &bench_signal(static_cast<std::size_t>(state.range(0)));
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return nullptr;
  }
}

std::string bench_signal_dir() {
  const char* dir = std::getenv("DRIFTLAB_BENCH_SIGNALS");
  return dir ? dir : "";
}

const BenchSignal& bench_signal(std::size_t n) {
  static std::mutex mutex;
  static std::map<std::size_t, std::unique_ptr<BenchSignal>> cache;
  std::lock_guard lock(mutex);
  auto& slot = cache[n];
  if (!slot) slot = std::make_unique<BenchSignal>(load(n));
  return *slot;
}

RegressionProblem regression_problem(std::size_t n) {
  const auto& signal = bench_signal(n);
  const Eigen::Index size = signal.temp_c.size();
  const auto half_window = static_cast<Eigen::Index>(std::max(1.0, 0.5 * signal.sample_rate_hz));
  RegressionProblem p{Eigen::MatrixXd(size, 2), signal.rate_rad_s};
  p.features.col(0) = signal.temp_c;
  for (Eigen::Index i = 0; i < size; ++i) {
    const Eigen::Index lo = std::max<Eigen::Index>(0, i - half_window);
    const Eigen::Index hi = std::min(size - 1, i + half_window);
    p.features(i, 1) = (signal.temp_c[hi] - signal.temp_c[lo]) / (signal.time_s[hi] - signal.time_s[lo]);
  }
  return p;
}

void run_regressor(benchmark::State& state, const std::string& plugin, const std::vector<std::string>& assignments) {
  RegressionProblem problem;
  try {
    problem = regression_problem(static_cast<std::size_t>(state.range(0)));
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  Registry registry;
  register_builtin_plugins(registry);
  const auto params = params_from_assignments(registry, plugin, assignments);
  for (auto _ : state) {
    auto regressor = registry.create_as<Regressor>({plugin, params});
    RunContext ctx;
    ctx.threads = 1;
    regressor->fit(problem.features, problem.target, ctx);
    benchmark::DoNotOptimize(regressor->predict(problem.features.topRows(1)));
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

}  // namespace driftlab::bench
