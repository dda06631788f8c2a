// Causal compensation benchmarks (issue 13), one core:
//   BM_CompensatePoly/N        CausalCompensator::step over N samples, cubic polynomial model
//   BM_CompensatePhysical/N    the same with lag, dT/dt and hysteresis terms (three filters, one exp
//                              per sample for the hysteresis path; exp(-dt/tau) cached for equal steps)
//   BM_CompensateStreamCommand/N  `driftlab compensate --stream` on an N-row CSV through a pipe
//                              (process start, parsing, formatting and writing included; wall time)
// Targets: >= 10 M samples/s for the library API, >= 1 M rows/s for the command.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <fstream>
#include <unistd.h>

#include "models/calibration/calibration_model.hpp"

namespace driftlab {
namespace {

calibration::CalibrationModel poly_model() {
  calibration::CalibrationModel m;
  m.reference_temp_c = 25.0;
  m.valid_min_c = -30.0;
  m.valid_max_c = 60.0;
  m.bias_rad_s = {4e-4, -1.1e-5, -1.4e-8, 3e-10};
  return m;
}

calibration::CalibrationModel physical_model() {
  auto m = poly_model();
  m.kind = calibration::ModelKind::Physical;
  m.lag_tau_s = 240.0;
  m.derivative_tau_s = 30.0;
  m.temperature_rate_rad_s_per_k_s = 3e-3;
  m.hysteresis_rad_s = -5e-5;
  m.hysteresis_width_k = 2.0;
  return m;
}

struct Record {
  Eigen::VectorXd t, rate, temp;
};

const Record& record(std::size_t n) {
  static std::map<std::size_t, Record> cache;
  auto& r = cache[n];
  if (r.t.size() == 0) {  // 100 Hz, an oven-like temperature swing with sensor noise
    r.t = Eigen::VectorXd::LinSpaced(static_cast<Eigen::Index>(n), 0.0, (static_cast<double>(n) - 1) * 0.01);
    r.temp.resize(r.t.size());
    r.rate.resize(r.t.size());
    for (Eigen::Index i = 0; i < r.t.size(); ++i) {
      r.temp[i] = 15.0 + 45.0 * std::sin(r.t[i] / 3000.0) + 0.01 * std::sin(1e3 * i);
      r.rate[i] = 1e-3 * std::cos(0.37 * i);
    }
  }
  return r;
}

void run(benchmark::State& state, const calibration::CalibrationModel& model) {
  const Record& r = record(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state) {
    calibration::CausalCompensator c(model);
    double sum = 0.0;
    for (Eigen::Index i = 0; i < r.t.size(); ++i) sum += c.step(r.t[i], r.rate[i], r.temp[i]);
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_CompensatePoly(benchmark::State& state) { run(state, poly_model()); }
void BM_CompensatePhysical(benchmark::State& state) { run(state, physical_model()); }

void BM_CompensateStreamCommand(benchmark::State& state) {
  const auto dir = std::filesystem::temp_directory_path() / ("driftlab_bench_stream_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto model = dir / "model.json", csv = dir / "in.csv";
  std::ofstream(model) << calibration::to_json_text(calibration::single_axis(physical_model()));
  {
    const Record& r = record(static_cast<std::size_t>(state.range(0)));
    std::ofstream out(csv);
    out << "t_s,rate_dps,temp_c\n";
    char line[96];
    for (Eigen::Index i = 0; i < r.t.size(); ++i) {
      std::snprintf(line, sizeof line, "%.2f,%.6f,%.2f\n", r.t[i], r.rate[i] * kDegPerRad, r.temp[i]);
      out << line;
    }
  }
  const std::string command = std::string(DRIFTLAB_EXE) + " compensate --model " + model.string() + " --stream < " +
                              csv.string() + " > /dev/null";
  for (auto _ : state) {
    if (std::system(command.c_str()) != 0) {
      state.SkipWithError("driftlab compensate --stream failed");
      break;
    }
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
  std::filesystem::remove_all(dir);
}

BENCHMARK(BM_CompensatePoly)->Arg(1'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CompensatePhysical)->Arg(1'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CompensateStreamCommand)->Arg(2'000'000)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

}  // namespace
}  // namespace driftlab
