#include "tools/bench/bench_signals.hpp"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>

#include "framework/csv.hpp"

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
    const auto got = f ? std::fread(s.rate_rad_s.data(), sizeof(double), static_cast<std::size_t>(s.rate_rad_s.size()), f) : 0;
    if (f) std::fclose(f);
    if (got != static_cast<std::size_t>(s.rate_rad_s.size())) throw std::runtime_error("cannot read " + f64.string());
    s.rate_rad_s *= 3.14159265358979323846 / 180.0;
    s.time_s = Eigen::VectorXd::LinSpaced(s.rate_rad_s.size(), 0.0, static_cast<double>(s.rate_rad_s.size() - 1) / 100.0);
    return s;
  }
  throw std::runtime_error("benchmark signal " + csv.string() + " (or .f64) not found; generate the signals with\n"
                           "  python3 ../shared/bench/gen_signals.py --out DIR\nand set DRIFTLAB_BENCH_SIGNALS=DIR");
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

}  // namespace driftlab::bench
